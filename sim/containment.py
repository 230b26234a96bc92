"""Containment: is every vehicle a decision depends on, and the AV itself, still inside the set it was proved safe
against? An observer of the simulator, checked every control step.

A decision (a plan, a step in lane, or the paper model's plan, measured the same way) is made from one snapshot;
under the drive's bounds (``spec.assumptions.world_bounds``) each vehicle of that snapshot is an interval that grows
with its lane's speeds (``spec.sound.reach_m``), and where the sensors cannot see, a phantom's interval covers what
may come from beyond. At every control step each vehicle's true position since the snapshot must be inside its own
interval, and each vehicle the decision knew must drive at a speed within its lane's bounds (the reach sets are
positions, but the safety specification's gaps depend on closing speeds: a vehicle ahead that brakes hard is inside
its interval for seconds after its speed left the bounds the proof assumed); a vehicle the decision did not know
(missed, occluded, respawned) must be inside a phantom's, or behind the AV in the oncoming lane (past it). Where
followers react (``Bounds.followers_react``), a same-direction vehicle behind the AV in its lane is assumed to follow
it (``spec.sound``: a rear-end collision is the follower's to avoid): one nearer than the safety specification allows
at its closing speed breaks that assumption; where they keep their speed, the model protects the AV from them
(``Conflict.BEHIND``) and they are held to their intervals like any other vehicle. The AV must be inside its envelope
(``spec.envelope.TRACKING``) around the executor's reference, its sideways move finished in the stated time. A
departure is a ``Breach``, recorded once per decision and vehicle with the bound it broke and by how much; an AV
envelope breach is an executor fault, which counts as inside the assumptions (an injected steering fault under way
does not: the simulator's attribution).

That check reads the truth: it is the simulator's bookkeeping (what broke, when, and whose a collision is), and it
never steers the AV. The AV's own monitor (``sim.driver.monitor.Monitor``, which ``Containment`` extends) sees what
its planner sees, each sweep's readings without identities: a reading that no vehicle's interval nor any phantom's
can explain, the sensing error allowed once more (the reading's own), is a breach the AV knows of, and that is what
ends a sound decision. A vehicle that leaves its bounds unseen (a speed outside them while still inside its interval,
a reading the sensors missed) goes on until the sensors show it; the run counts those decisions (``unseen``).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

from sim.driver.monitor import ROUNDING_M, Breach, BreachKind, Monitor, apart, outside
from sim.driver.readings import Reading
from sim.faults import GHOST_BODY
from sim.scene import Scene
from sim.vehicle import KinematicCar, Pose
from spec.grid import Grid
from spec.lanes import Lane
from spec.physical import CAR, ROAD
from spec.safety import SAFETY
from spec.scenario import Scenario
from spec.sound import Sound, Vehicle, reach_m

#: Breach records kept per run (the counts are exact beyond it).
MAX_RECORDS = 200
#: A speed this close outside its bounds is inside them (``sim.driver.monitor.ROUNDING_M`` for speeds): the paper's
#: world sets every vehicle's speed to the bound's one value, exactly.
ROUNDING_MPS = 1e-9


@dataclass(slots=True)
class ContainmentReport:
    """One run's containment figures: breaches by kind, the first ``MAX_RECORDS`` of them, and the time checked."""

    checked_s: float = 0.0  # simulated time under a decision's containment
    breached_s: float = 0.0  # of it, time after a breach of that decision (until the next decision)
    by_kind: Counter[str] = field(default_factory=Counter)
    breaches: list[Breach] = field(default_factory=list)

    @property
    def count(self) -> int:
        return sum(self.by_kind.values())

    def add(self, breach: Breach) -> None:
        self.by_kind[breach.kind.value] += 1
        if len(self.breaches) < MAX_RECORDS:
            self.breaches.append(breach)

    def to_json(self) -> dict[str, Any]:
        return {"checked_s": round(self.checked_s, 1), "breached_s": round(self.breached_s, 1),
                "by_kind": dict(self.by_kind), "breaches": [b.to_json() for b in self.breaches]}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> ContainmentReport:
        return cls(data["checked_s"], data["breached_s"], Counter(data["by_kind"]),
                   [Breach.from_json(b) for b in data["breaches"]])


class Containment(Monitor):
    """The sets one decision was made against, from its snapshot (the AV's own ``Monitor``), with the truth held
    against them: the breaches found since."""

    def __init__(self, decision: int, sound: Sound, scenario: Scenario, seen: tuple[Reading, ...], grid: Grid,
                 av_x_m: float, t_s: float, cars: Iterable[KinematicCar],
                 read: tuple[Reading, ...] | None = None) -> None:
        super().__init__(decision, sound, scenario, seen, grid, av_x_m, t_s, read)
        self.tracking = sound.tracking
        cars = list(cars)
        truth_m = {car.body: car.x_m - av_x_m for car in cars}  # the bookkeeping only
        own = _own_readings(seen, truth_m)
        #: the vehicle the decision knew each body as: the one its own reading made
        self.tracked = {reading.body: vehicle for reading, vehicle in self.placed if own.get(reading.body) is reading}
        # a reading of no vehicle (a ghost a fault made, or one the tracker holds), or a vehicle's second reading away
        # from it (a fake gap's displaced copy held beside the vehicle's own kept track): the snapshot broke the sensing
        # assumption (every reading within the error bound of a vehicle), whatever it is planned around
        self.ghosts = [r for r in seen if r.body == GHOST_BODY]
        error_m = 0.0 if sound.sensed_sets else self.bounds.sensing_error_m  # a set holds the error
        self.misread = [(r, miss) for r in seen if r.body in own and r is not own[r.body]
                        and (miss := abs(apart(*r.interval_m, truth_m[r.body] - error_m, truth_m[r.body] + error_m)))]
        self.generation = {car.body: car.respawns for car in cars}  # a respawned car is a new vehicle
        self.breached: dict[int, Breach] = {}  # body (-1: the AV) -> its first breach under this decision
        self.ended = False  # the decision has ended (its unseen breaches counted: ``unseen``)

    def _known(self, car: KinematicCar) -> Vehicle | None:
        """The vehicle the decision knew ``car`` as (None: unknown)."""
        return self.tracked.get(car.body) if car.respawns == self.generation.get(car.body) else None

    @staticmethod
    def _name(lane: Lane, known: Vehicle | None) -> str:
        return known.name if known else f"unknown {lane.value}-lane vehicle"

    def check(self, t_s: float, km: float, av: Pose, left: Iterable[KinematicCar], oncoming: Iterable[KinematicCar],
              doing: str, sensed: Callable[[KinematicCar], bool]) -> list[Breach]:
        """The new breaches of every vehicle at ``t_s`` (the drive's clock); each vehicle breaches at most once. A
        vehicle the decision did not know counts only once ``sensed`` says the sensors see it (one hidden behind
        another is no vehicle a decision could have known)."""
        elapsed = t_s - self.t0_s
        out = []
        if self.ghosts and GHOST_BODY not in self.breached:
            ghost = self.ghosts[0]
            out.append(self._breach(Breach(self.decision, km, t_s, f"a reading of no vehicle ({ghost.lane.value} "
                                           f"lane, {ghost.dx_m:+.1f} m)", GHOST_BODY, BreachKind.SENSING, 0.0, doing)))
        for r, miss in self.misread:
            if r.body not in self.breached:
                out.append(self._breach(Breach(self.decision, km, t_s, f"a second reading of vehicle {r.body} ("
                                               f"{r.lane.value} lane, {r.dx_m:+.1f} m)", r.body, BreachKind.SENSING,
                                               miss, doing)))
        av_in_left = av.y_m >= 0
        reach: dict[int, tuple[float, float]] = {}  # each interval's reach at ``elapsed``, once per check
        for lane, cars in ((Lane.LEFT, left), (Lane.RIGHT, oncoming)):
            for car in cars:
                if car.body in self.breached:
                    continue
                if lane is Lane.LEFT and av_in_left and car.x_m < av.x_m and self.bounds.followers_react:
                    gap_m = av.x_m - car.x_m - CAR.length_m
                    closing_mps = car.velocity_mps - av.along_mps
                    if SAFETY.violated(gap_m, closing_mps):
                        out.append(self._breach(Breach(self.decision, km, t_s, f"follower ({car.body})", car.body,
                                                       BreachKind.FOLLOWER,
                                                       SAFETY.required_gap_m(closing_mps) - gap_m, doing)))
                        continue
                known = self._known(car)
                miss = self._miss(lane, car, known, av, elapsed, reach)
                if miss == 0.0:
                    if known is not None and (speeding := self._speed(lane, car, known, elapsed, t_s, km, doing)):
                        out.append(speeding)
                    continue
                if known is None and not sensed(car):
                    continue
                if known is None:
                    kind = BreachKind.APPEARED
                elif elapsed <= 0.0:
                    kind = BreachKind.SENSING
                else:  # behind the interval's slow end: too slow in the left lane, too fast in the oncoming one
                    slow = (miss < 0) == (lane is Lane.LEFT)
                    kind = BreachKind.TOO_SLOW if slow else self._fast_kind(known, elapsed, car.x_m - self.x0_m)
                out.append(self._breach(Breach(self.decision, km, t_s, self._name(lane, known), car.body, kind,
                                               abs(miss), doing)))
        return out

    def _miss(self, lane: Lane, car: KinematicCar, known: Vehicle | None, av: Pose, elapsed_s: float,
              reach: dict[int, tuple[float, float]]) -> float:
        """How far ``car``, known to the decision as ``known`` (None: unknown, any of its lane's phantoms), is outside
        every interval it must be inside ``elapsed_s`` after the snapshot (0: inside one, or an oncoming vehicle the AV
        has passed, of which no condition speaks). ``reach`` holds the intervals' reaches at ``elapsed_s`` already
        computed (by ``id``: the decision's vehicles live as long as it does)."""
        if known is None and lane is Lane.RIGHT and car.x_m < av.x_m - CAR.length_m:
            return 0.0
        dx = car.x_m - self.x0_m
        misses = []
        for v in [known] if known else self.phantoms[lane]:
            ends = reach.get(id(v))
            if ends is None:
                ends = reach[id(v)] = reach_m(self.assumed(v, elapsed_s), self.bounds, elapsed_s)
            misses.append(outside(dx, *ends))
        return min(misses, key=abs, default=0.0)

    def _fast_kind(self, known: Vehicle, elapsed_s: float, dx_m: float) -> BreachKind:
        """A known vehicle beyond its interval's fast end: ``accelerated while overtaken`` where only the held
        speed of a passing window puts it there (``assumed``), else ``too fast``."""
        if self.assumed(known, elapsed_s) is known or dx_m > reach_m(known, self.bounds, elapsed_s)[1] + ROUNDING_M:
            return BreachKind.TOO_FAST
        return BreachKind.ACCELERATED

    def hidden(self, t_s: float, km: float, av: Pose, lane: Lane, car: KinematicCar, doing: str) -> Breach | None:
        """The breach of a vehicle the decision did not know and the sensors do not show, where no phantom could be:
        for the attribution of an encounter only, never recorded (``check`` counts an unknown vehicle once sensed: one
        hidden behind another is no vehicle a decision could have known). A vehicle the sensing assumption says the
        AV would have sensed broke it all the same, and one touching the AV is one no ray reaches."""
        if self._known(car) is not None:
            return None
        miss = self._miss(lane, car, None, av, t_s - self.t0_s, {})
        if miss == 0.0:
            return None
        return Breach(self.decision, km, t_s, f"{self._name(lane, None)} the sensors did not show", car.body,
                      BreachKind.APPEARED, abs(miss), doing)

    def _speed(self, lane: Lane, car: KinematicCar, known: Vehicle, elapsed_s: float, t_s: float, km: float,
               doing: str) -> Breach | None:
        """``car``'s breach of its speed bounds, if it drives outside them (its true speed along the lane): its lane's,
        or, for a vehicle whose speed was measured, what its own dynamics allow ``elapsed_s`` after the snapshot."""
        bounds = self.bounds.speeds(lane)
        low, high = bounds.low_mps, bounds.high_mps
        assumed = self.assumed(known, max(0.0, elapsed_s))
        if assumed.dynamics is not None:
            low, high = assumed.dynamics.speeds_mps(max(0.0, elapsed_s))
        along_mps = car.velocity_mps if lane is Lane.LEFT else -car.velocity_mps
        miss = outside(along_mps, low, high, ROUNDING_MPS)
        if miss == 0.0:
            return None
        if known.dynamics is not None and elapsed_s <= 0.0:  # outside what was measured at the snapshot itself
            kind = BreachKind.SENSING
        elif miss < 0:
            kind = BreachKind.TOO_SLOW
        else:  # beyond the held speed, within what its own dynamics allow: it sped up while being overtaken
            physical = known.dynamics.speeds_mps(elapsed_s)[1] if known.dynamics is not None else high
            kind = BreachKind.ACCELERATED if assumed is not known and along_mps <= physical + ROUNDING_MPS else \
                BreachKind.TOO_FAST
        return self._breach(Breach(self.decision, km, t_s, known.name, car.body, kind, abs(miss), doing, speed=True))

    def check_av(self, t_s: float, km: float, av: Pose, x_ref_m: float, v_ref_mps: float, lane_due: Lane | None,
                 doing: str) -> Breach | None:
        """The AV's breach of its envelope, if new: off its reference by more than the stated tracking, or not
        wholly in ``lane_due`` once its sideways move should be over."""
        if -1 in self.breached:
            return None
        t = self.tracking
        errors = [(abs(av.x_m - x_ref_m) - t.position_m, "position"), (abs(av.along_mps - v_ref_mps) - t.speed_mps,
                                                                          "speed")]
        if lane_due is not None:
            errors.append((abs(av.y_m - Scene.lane_y(lane_due)) - (ROAD.lane_width_m - CAR.width_m) / 2, "sideways"))
        by, what = max(errors)
        if by <= 0:
            return None
        return self._breach(Breach(self.decision, km, t_s, f"the AV ({what})", -1, BreachKind.AV_ENVELOPE, by,
                                   doing, speed=what == "speed"))

    def _breach(self, breach: Breach) -> Breach:
        self.breached[breach.body] = breach
        return breach

    def unseen(self) -> bool:
        """Whether a vehicle broke an assumption that ends a decision (the truth) while the AV's own monitor never
        sensed a breach: a decision that went on past a breach its sensors did not show."""
        return self.world_breached() and self.sensed is None

    def world_breached(self) -> bool:
        """Whether a vehicle (not the AV) has broken an assumption under this decision that ends it."""
        return any(body != -1 and b.kind.ends_decision for body, b in self.breached.items())


def _own_readings(seen: Iterable[Reading], truth_m: dict[int, float]) -> dict[int, Reading]:
    """Each vehicle's own reading among the snapshot's (the bookkeeping: bodies and the truth): of a vehicle read more
    than once, the one nearest where it is."""
    own: dict[int, Reading] = {}
    for r in seen:
        if r.body in truth_m and (r.body not in own or abs(r.dx_m - truth_m[r.body]) < abs(own[r.body].dx_m
                                                                                          - truth_m[r.body])):
            own[r.body] = r
    return own
