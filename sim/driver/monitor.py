"""The AV's own monitor of a decision (``Monitor``): the sets its vehicles were proved inside, from the decision's
snapshot (no identities, no truth), and whether a sweep's readings leave them (``Monitor.sense``), which ends a
sound decision; and the paper model's re-planning rule on the same readings (``Sighting``).

A decision is made from one snapshot; under the drive's bounds (``spec.assumptions.world_bounds``) each vehicle of
that snapshot is an interval that grows with its lane's speeds (``spec.sound.reach_m``; a vehicle whose speed was
measured, with its own dynamics), and where the sensors cannot see, a phantom's interval covers what may come from
beyond. A reading that no vehicle's interval nor any phantom's can explain, the sensing error allowed once more (the
reading's own), is a breach the AV knows of; while none is, the next snapshot's readings are narrowed to what they
and the sets share (``Monitor.refine``). The simulator's bookkeeping holds every vehicle's truth against the same
sets (``sim.containment.Containment``, which extends this monitor).
"""

from __future__ import annotations

import enum
import math
from collections import Counter
from collections.abc import Iterable
from dataclasses import asdict, dataclass, replace
from typing import Any

from sim.driver.discretiser import discretise, in_window, reading_cell
from sim.driver.readings import Reading
from spec.actions import Action
from spec.assumptions import Bounds
from spec.errors import ScenarioError
from spec.grid import Grid
from spec.lanes import Lane
from spec.physical import CAR
from spec.scenario import Scenario
from spec.sound import Sound, Vehicle, held_vehicle, held_windows_s, reach_m, slowest_ahead_mps, vehicles

#: A vehicle this close outside its interval is inside it: floating-point rounding of positions a kilometre from the
#: origin (~1e-13 m), not motion. The paper's world makes it matter: exact sensing and every vehicle at 7 m/s give
#: intervals of no width, which every vehicle left by 1e-12 m within a control step (each decision ended by a breach).
ROUNDING_M = 1e-6
#: The ``body`` of a breach the AV's own monitor found: a reading, no vehicle's identity (the AV is -1).
SENSED_BODY = -4


class BreachKind(enum.Enum):
    """Which assumption a breach broke."""

    #: behind its interval's slow end, or driving slower than its lane's lowest speed (a vehicle whose speed was
    #: measured: than braking at b_max from its interval allows)
    TOO_SLOW = "too slow"
    #: beyond its interval's fast end, or driving faster than its lane's highest speed (a vehicle whose speed was
    #: measured: than speeding up at a_max from its interval allows)
    TOO_FAST = "too fast"
    #: faster, or farther, than a measured same-direction vehicle may be while the AV is in the passing lane under
    #: ``Overtaken.NO_ACCELERATION`` (it sped up while being overtaken), within what its own dynamics allow
    ACCELERATED = "accelerated while overtaken"
    SENSING = "sensing error"  # outside its interval at the snapshot itself (sensed farther off than the error
    # bound; a measured speed: a range-rate reading beyond its error bound), or a reading of no vehicle (a ghost)
    APPEARED = "appeared"  # a vehicle the decision did not know, where no phantom could be
    FOLLOWER = "follower too close"  # one behind the AV in its lane nearer than the safety specification allows
    AV_ENVELOPE = "AV envelope"  # the AV off its reference by more than its stated tracking, or its sideways move late

    @property
    def inside(self) -> bool:
        """Whether a collision after this breach still counts as inside the assumptions (the executor's fault)."""
        return self is BreachKind.AV_ENVELOPE

    @property
    def ends_decision(self) -> bool:
        """Whether the sound model re-plans on it: not on a follower (avoiding the AV is the follower's task, and
        braking would make it worse), on every other breach."""
        return self is not BreachKind.FOLLOWER


@dataclass(frozen=True, slots=True)
class Breach:
    """One vehicle (or the AV) outside its set: when, which bound, by how much, during what."""

    decision: int
    km: float
    t_s: float  # the drive's clock
    vehicle: str
    body: int  # -1: the AV
    kind: BreachKind
    by_m: float  # beyond the bound: metres, or m/s for a speed (``speed``)
    doing: str
    speed: bool = False  # whether the bound broken is a speed (a vehicle's or the AV's), not a position
    sensed: bool = False  # found by the AV's own monitor in a sweep's readings (``Monitor.sense``), not the truth

    @property
    def size(self) -> str:
        """How far beyond the bound, with its unit."""
        return f"{self.by_m:.1f} {'m/s' if self.speed else 'm'}"

    def to_json(self) -> dict[str, Any]:
        return {**asdict(self), "kind": self.kind.value, "km": round(self.km, 3), "t_s": round(self.t_s, 2),
                "by_m": round(self.by_m, 2)}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> Breach:
        return cls(**{**data, "kind": BreachKind(data["kind"])})


class Monitor:
    """The sets one decision was made against, from its snapshot as its planner got it, and the first reading the AV
    sensed outside them (``sensed``)."""

    def __init__(self, decision: int, sound: Sound, scenario: Scenario, seen: tuple[Reading, ...], grid: Grid,
                 av_x_m: float, t_s: float, read: tuple[Reading, ...] | None = None) -> None:
        self.decision, self.bounds = decision, sound.bounds
        self.x0_m, self.t0_s = av_x_m, t_s
        self.lane, self.sound = scenario.lane, sound
        #: the decision's passing windows (``passing``): measured same-direction vehicles hold their speed in them
        self.windows_s: tuple[tuple[float, float], ...] = ()
        #: each reading in the window with the vehicle it makes, and what may explain a reading of each lane
        #: (``sense``): the vehicles the decision knew, then the phantoms
        found, self.placed, self.explaining = _explained(scenario, seen, grid, sound)
        self.phantoms = {lane: [v for v in found if v.index is None and v.lane is lane] for lane in Lane}
        #: what the next snapshot is narrowed against (``refine``): the vehicles as the snapshot ``read`` them, each
        #: within the sensing error of its reading, not the sets a narrowed snapshot made of them (a reading beyond
        #: the error bound narrows one decision's sets, never every later one's)
        self.read_explaining = self.explaining
        if read is not None and sound.sensed_sets:
            try:
                raw = discretise(read, scenario.lane, grid, measured=True)
            except ScenarioError:
                raw = None
            if raw is not None:
                self.read_explaining = _explained(raw, read, grid, replace(sound, sensed_sets=False))[2]
        self.sensed: Breach | None = None  # the first reading the AV's own monitor could not explain (``sense``)
        #: the speed the decision's minimal-risk manoeuvre brakes to, as its proof took it (``slowest_ahead_mps``: a
        #: standstill where a vehicle's speed was measured)
        self.hold_floor_mps = slowest_ahead_mps(sound, found)

    def shift_x(self, dx_m: float) -> None:
        """The world was re-centred by ``dx_m``."""
        self.x0_m += dx_m

    def passing(self, actions: tuple[Action, ...]) -> None:
        """The decision executes ``actions``: under ``Overtaken.NO_ACCELERATION`` its proof took every measured
        same-direction vehicle not to speed up while the AV is in the passing lane (``passing_windows_s``)."""
        self.windows_s = held_windows_s(self.sound, self.lane, actions)

    def assumed(self, v: Vehicle, elapsed_s: float) -> Vehicle:
        """``v`` as the decision's proof took it ``elapsed_s`` after the snapshot: within a passing window, a measured
        same-direction vehicle that has not sped up since the window began (``passing``)."""
        return held_vehicle(v, self.windows_s, elapsed_s)

    def sense(self, t_s: float, km: float, av_x_m: float, readings: Iterable[Reading], doing: str,
              followed: bool = False) -> Breach | None:
        """The AV's own monitor, on one sweep's readings as its planner gets them (no identities, no truth): the first
        reading whose interval (a kept track's spread, widened by the sensing error bound: the reading's own error)
        meets no interval of its lane at ``t_s``, neither a vehicle's the decision knew nor a phantom's, if new. An
        oncoming reading the AV has passed is no vehicle any condition speaks of. Its kind is read from the nearest
        interval: behind a known vehicle's (``too slow`` in the left lane), beyond it (``too fast``; ``accelerated
        while overtaken`` where only a passing window's held speed puts it there), or none known near
        (``appeared``). With ``followed`` (the AV in the left lane, or moving out of it) a left-lane reading behind the
        AV's centre is a vehicle that follows it, which cannot pass it in its lane, so every condition a decision
        proved bounds it from ahead: one behind its interval (``too slow``) breaks none of them and is not acted on
        (the truth's bookkeeping, ``Containment.check``, still counts it)."""
        if self.sensed is not None:
            return None
        elapsed, shift_m = t_s - self.t0_s, av_x_m - self.x0_m
        for r in readings:
            if r.lane is Lane.RIGHT and r.dx_m < -CAR.length_m:
                continue
            misses = [(_miss_m(r, self.assumed(v, elapsed), self.bounds, shift_m, elapsed), v)
                      for v in self.explaining[r.lane]]
            if any(miss == 0.0 for miss, _ in misses):
                continue
            miss, nearest = min(misses, key=lambda m: abs(m[0]), default=(math.inf, None))
            if nearest is None or nearest.index is None or not math.isfinite(miss):
                kind = BreachKind.APPEARED
            elif (miss < 0) == (r.lane is Lane.LEFT):
                kind = BreachKind.TOO_SLOW
            else:
                held = self.assumed(nearest, elapsed) is not nearest
                kind = BreachKind.ACCELERATED if held and _miss_m(r, nearest, self.bounds, shift_m, elapsed) == 0.0 \
                    else BreachKind.TOO_FAST
            if followed and kind is BreachKind.TOO_SLOW and r.lane is Lane.LEFT and r.dx_m < 0:
                continue  # a follower farther behind than its bounds allow
            self.sensed = Breach(self.decision, km, t_s, f"a sensed {r.lane.value}-lane reading at {r.dx_m:+.1f} m",
                                 SENSED_BODY, kind, abs(miss) if math.isfinite(miss) else 0.0, doing, sensed=True)
            return self.sensed
        return None


    def refine(self, readings: tuple[Reading, ...], t_s: float, av_x_m: float) -> tuple[Reading, ...] | None:
        """A sweep's readings (the AV at ``av_x_m`` at ``t_s``) that this decision's sets explain (``sense`` found
        none outside them) as sets each vehicle is known to be in, the sensing error held
        (``spec.sound.Sound.sensed_sets``): where the reading's own error and the sets it meets share (``known_m``),
        the sets of the vehicles as this decision's snapshot read them (``read_explaining``), grown by the bounds
        since. Every vehicle of that snapshot was read within the error, or is beyond a phantom's edge, or has
        ``appeared`` (a breach: ``spec.assumptions``), and moves within its bounds, so while every assumption holds
        each vehicle read now is in both (SPOT's set-based prediction refined by a measurement). A vehicle read is one
        vehicle: where two readings meet its set, one of them may be a vehicle hidden at that snapshot, and neither
        is narrowed. A reading so narrowed by nothing, or one that may be an oncoming vehicle the AV has passed, is
        its interval widened by the error. A noisy reading nearer than the sets then asks for no more room than the
        proof holds. None: no reading narrowed, the readings as read."""
        elapsed, shift_m, error_m = t_s - self.t0_s, av_x_m - self.x0_m, self.bounds.sensing_error_m
        sets = {lane: [(v, _shifted(reach_m(self.assumed(v, elapsed), self.bounds, elapsed), -shift_m))
                       for v in self.read_explaining[lane]] for lane in Lane}
        wide = [(r.interval_m[0] - error_m, r.interval_m[1] + error_m) for r in readings]
        met: list[list[tuple[Vehicle, tuple[float, float]]]] = []
        claims: Counter[tuple[Lane, int | None]] = Counter()  # readings meeting each known vehicle's set
        for r, w in zip(readings, wide, strict=True):
            passed = r.lane is Lane.RIGHT and r.dx_m < error_m - CAR.length_m
            met.append([] if passed else [(v, m) for v, m in sets[r.lane] if known_m(w, [m]) is not None])
            claims.update((v.lane, v.index) for v, _ in met[-1] if v.index is not None)
        out, narrower = [], False
        for r, w, meeting in zip(readings, wide, met, strict=True):
            alone = all(v.index is None or claims[(v.lane, v.index)] == 1 for v, _ in meeting)
            a, b = (known_m(w, [m for _, m in meeting]) or w) if meeting and alone else w
            narrower = narrower or a > w[0] + ROUNDING_M or b < w[1] - ROUNDING_M
            dx_m = min(max(r.dx_m, a), b)
            out.append(replace(r, dx_m=dx_m, spread_m=(dx_m - a, b - dx_m)))
        return tuple(out) if narrower else None


def _shifted(interval_m: tuple[float, float], dx_m: float) -> tuple[float, float]:
    return interval_m[0] + dx_m, interval_m[1] + dx_m


class Sighting:
    """The vehicles one snapshot showed, as the planner knows them (readings: a lane and a distance, no identity), for
    the paper's re-planning rule: re-plan when "new surrounding vehicles were sensed". A later reading is a vehicle
    sensed anew when no reading of the snapshot can explain it under ``bounds``: that reading's interval (the sensing
    error allowed), grown by its lane's speeds since (``spec.sound.reach_m``), meets none of the new reading's (its
    own error allowed). A vehicle read at the snapshot and missed since explains nothing extra; one hidden then and
    come out (of the oncoming lane's stretch a left-lane vehicle hid, ``sim.sensors.oncoming_view_m``), or entered
    the sensors' range, is new."""

    def __init__(self, readings: Iterable[Reading], bounds: Bounds, av_x_m: float, t_s: float) -> None:
        self.bounds, self.x0_m, self.t0_s = bounds, av_x_m, t_s
        error_m = bounds.sensing_error_m
        self.known = {lane: [Vehicle(lane, None, r.interval_m[0] - error_m, r.interval_m[1] + error_m, "")
                             for r in readings if r.lane is lane] for lane in Lane}

    def shift_x(self, dx_m: float) -> None:
        """The world was re-centred by ``dx_m``."""
        self.x0_m += dx_m

    def new(self, readings: Iterable[Reading], av_x_m: float, t_s: float) -> bool:
        """Whether a reading of this sweep (the AV at ``av_x_m`` at ``t_s``) is a vehicle the snapshot did not show."""
        elapsed, shift_m = t_s - self.t0_s, av_x_m - self.x0_m
        for r in readings:
            if not any(_miss_m(r, v, self.bounds, shift_m, elapsed) == 0.0 for v in self.known[r.lane]):
                return True
        return False


def _explained(scenario: Scenario, seen: tuple[Reading, ...], grid: Grid, sound: Sound) -> tuple[
        tuple[Vehicle, ...], list[tuple[Reading, Vehicle]], dict[Lane, list[Vehicle]]]:
    """A snapshot's vehicles (``seen`` made ``scenario``), each reading in the window with the vehicle it makes (a
    lane's cells in the window, nearest first, are its scenario's vehicles in order; readings in one cell: one hull,
    one vehicle), and what may explain a later reading of each lane: the vehicles the readings make, then the
    phantoms."""
    found = vehicles(scenario.lane, scenario.left_lane, scenario.right_lane, grid, sound, scenario.left_m,
                     scenario.right_m, scenario.left_mps, scenario.right_mps)
    by_index = {(v.lane, v.index): v for v in found if v.index is not None}
    placed: list[tuple[Reading, Vehicle]] = []
    for lane in Lane:
        readings = sorted((r for r in seen if r.lane is lane), key=lambda r: r.dx_m)
        cells = [(c, r) for r in readings if in_window(c := reading_cell(r, scenario.lane, grid), grid)]
        order = sorted({c for c, _ in cells})
        placed += [(reading, by_index[(lane, order.index(cell))]) for cell, reading in cells]
    read = dict.fromkeys(v for _, v in placed)  # the vehicles the snapshot's readings make: what the AV knows
    explaining = {lane: [*(v for v in read if v.lane is lane),
                         *(v for v in found if v.index is None and v.lane is lane)] for lane in Lane}
    return found, placed, explaining


def known_m(read_m: tuple[float, float], sets_m: list[tuple[float, float]]) -> tuple[float, float] | None:
    """Where a vehicle can be that a reading puts within ``read_m`` (its interval widened by the sensing error) and
    that is inside one of ``sets_m``: the hull of what they share (None: nothing; touching within ``ROUNDING_M``
    shares a point)."""
    lo, hi = read_m
    shared = [(max(lo, low), min(hi, high)) for low, high in sets_m]
    shared = [(a, max(a, b)) for a, b in shared if a <= b + ROUNDING_M]
    if not shared:
        return None
    return min(a for a, _ in shared), max(b for _, b in shared)


def _miss_m(r: Reading, v: Vehicle, bounds: Bounds, shift_m: float, elapsed_s: float) -> float:
    """How far reading ``r`` (its interval moved by ``shift_m`` into the snapshot's frame, widened by the sensing
    error: the reading's own) lies outside where ``v`` can be ``elapsed_s`` after the snapshot: 0 where they meet."""
    error_m, (lo, hi) = bounds.sensing_error_m, r.interval_m
    return apart(lo + shift_m - error_m, hi + shift_m + error_m, *reach_m(v, bounds, elapsed_s))


def apart(lo: float, hi: float, low: float, high: float) -> float:
    """How far ``[lo, hi]`` lies outside ``[low, high]``: negative below, positive above, 0 where they meet."""
    return outside(hi, low, math.inf) if hi < low else outside(lo, -math.inf, high)


def outside(x: float, low: float, high: float, rounding: float = ROUNDING_M) -> float:
    """How far ``x`` is outside ``[low, high]``: negative below, positive above, 0 inside (or within ``rounding``
    of it)."""
    miss = x - low if x < low else x - high if x > high else 0.0
    return 0.0 if abs(miss) <= rounding else miss
